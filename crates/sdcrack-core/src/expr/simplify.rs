//! Simplifying constructors of the expression tree: sums, products, powers and function
//! applications that fold constants and drop neutral terms (`0*a -> 0`, `1*a -> a`,
//! `a + 0 -> a`) as they are built; what the derivative is made of.

use super::tree::{Fn1, Node};
use super::vm::literal_int;

pub(super) fn num(v: f64) -> Node {
    Node::Num(v)
}

pub(super) fn is_num(n: &Node, v: f64) -> bool {
    matches!(n, Node::Num(w) if *w == v)
}

pub(super) fn neg(a: Node) -> Node {
    match a {
        Node::Num(v) => Node::Num(-v),
        Node::Neg(b) => *b,
        other => Node::Neg(Box::new(other)),
    }
}

/// A chain being flattened (a sum's terms flagged when negated, a product's factors flagged when
/// divided): its operands are visited left to right, depth first, a nested chain of the same
/// kind spliced in place with its flags combined (`−(a − b)` gives −a, +b) and an operand pushed
/// back visited next; those the caller does not fold away are kept, in visiting order. The
/// explicit stack keeps deep trees off the call stack.
struct Flattening {
    /// The operands still to visit, the next one last.
    pending: Vec<(bool, Node)>,
    /// The operands kept so far.
    kept: Vec<(bool, Node)>,
}

impl Flattening {
    fn new(chain: Vec<(bool, Node)>) -> Self {
        Flattening {
            pending: chain.into_iter().rev().collect(),
            kept: Vec::new(),
        }
    }

    /// The next operand with its flag, `None` once all are visited.
    fn pop(&mut self) -> Option<(bool, Node)> {
        self.pending.pop()
    }

    /// Visits `node` next, with the flag `flag`.
    fn push(&mut self, flag: bool, node: Node) {
        self.pending.push((flag, node));
    }

    /// Visits the operands of the nested chain `inner` next, in order, each with its flag
    /// xor-ed with the chain's own `flag`.
    fn splice(&mut self, flag: bool, inner: Vec<(bool, Node)>) {
        for (f, n) in inner.into_iter().rev() {
            self.pending.push((flag ^ f, n));
        }
    }

    /// Keeps `node` with its flag as an operand of the flattened chain.
    fn keep(&mut self, flag: bool, node: Node) {
        self.kept.push((flag, node));
    }
}

/// Sum with flattening, zero removal and folding of the numeric terms.
pub(super) fn add(terms: Vec<(bool, Node)>) -> Node {
    let mut c = 0.0f64;
    let mut operands = Flattening::new(terms);
    while let Some((s, t)) = operands.pop() {
        match t {
            Node::Num(v) if (c + if s { -v } else { v }).is_finite() => {
                c += if s { -v } else { v };
            }
            Node::Sum(inner) => operands.splice(s, inner),
            Node::Neg(inner) => operands.push(!s, *inner),
            other => operands.keep(s, other),
        }
    }
    let mut out = operands.kept;
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
pub(super) fn mul(factors: Vec<(bool, Node)>) -> Node {
    let mut c = 1.0f64;
    let mut operands = Flattening::new(factors);
    while let Some((d, f)) = operands.pop() {
        match f {
            Node::Num(v) if !d && v == 0.0 => return num(0.0),
            Node::Num(v) if (if d { c / v } else { c * v }).is_finite() && v != 0.0 => {
                c = if d { c / v } else { c * v };
            }
            Node::Prod(inner) => operands.splice(d, inner),
            Node::Neg(inner) => {
                c = -c;
                operands.push(d, *inner);
            }
            other => operands.keep(d, other),
        }
    }
    let mut out = operands.kept;
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

pub(super) fn pow(a: Node, b: Node) -> Node {
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

pub(super) fn f1(f: Fn1, a: Node) -> Node {
    if let Node::Num(v) = a {
        let r = f.apply(v);
        if r.is_finite() {
            return num(r);
        }
    }
    Node::F1(f, Box::new(a))
}

pub(super) fn select(a: Node, b: Node, c: Node, d: Node) -> Node {
    if c == d {
        return c;
    }
    Node::Select(Box::new([a, b, c, d]))
}
