//! The stack program an [`Expr`](super::Expr) is compiled to, and its evaluation: one
//! instruction per tree node in post-order, literal integer exponents as `powi`, every
//! operation the same f64 operation as the tree's definition.

use super::tree::{Fn1, Fn2, Node};

#[derive(Clone, Copy, Debug)]
pub(super) enum Op {
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
pub(super) fn literal_int(n: &Node) -> Option<i32> {
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
pub(super) fn compile(n: &Node, code: &mut Vec<Op>) -> usize {
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

pub(super) fn run(code: &[Op], st: &mut [f64], x: f64, y: f64) -> f64 {
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
