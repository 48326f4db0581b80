//! Symbolic differentiation of the expression tree by `x` or `y`: sum, product, power and
//! chain rules, built with the simplifying constructors; `min`/`max` differentiate to a
//! select of the active argument's derivative.

use super::simplify::{add, f1, is_num, mul, neg, num, pow, select};
use super::tree::{is_const, Fn1, Fn2, Node, Var};

/// Product rule for a plain product `f_0 * f_1 * ... * f_n`.
pub(super) fn product_rule(fs: &[Node], var: Var) -> Node {
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
pub(super) fn deriv(n: &Node, var: Var) -> Node {
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
pub(super) fn deriv_sum(ts: &[(bool, Node)], var: Var) -> Node {
    add(ts.iter().map(|(s, t)| (*s, deriv(t, var))).collect())
}

#[inline(never)]
pub(super) fn deriv_prod(fs: &[(bool, Node)], var: Var) -> Node {
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
pub(super) fn deriv_pow(a: &Node, b: &Node, var: Var) -> Node {
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
pub(super) fn deriv_f1(f: Fn1, a: &Node, var: Var) -> Node {
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
pub(super) fn deriv_f2(f: Fn2, a: &Node, b: &Node, var: Var) -> Node {
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
pub(super) fn deriv_select(s: &[Node; 4], var: Var) -> Node {
    let [a, b, c, d] = s;
    select(a.clone(), b.clone(), deriv(c, var), deriv(d, var))
}
