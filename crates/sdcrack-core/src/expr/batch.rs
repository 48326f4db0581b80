//! Several expressions evaluated together over many points ([`ExprBatch`]).
//!
//! The error norms evaluate u, ∂u/∂x, ∂u/∂y and f at every quadrature point; the derivatives are
//! symbolic and repeat most of u's subexpressions (for the open crack's `Im sqrt(z² − 1/4)`, the
//! square roots and both `atan2`). Here the trees are lowered together into one register program
//! in which every distinct subexpression is one instruction (hash-consing), and each instruction
//! runs over a batch of points before the next, so the dispatch is paid once per batch instead of
//! once per point. Every value is computed by the same f64 operations, on the same operands and in
//! the same order, as [`Expr::eval`]: the results are bit for bit those of the stack program.

use super::expression::Expr;
use super::tree::{Fn1, Fn2, Node};
use super::vm::literal_int;
use std::collections::HashMap;

/// Points evaluated per pass over the program.
const LANES: usize = 64;

/// One instruction; operands are indices of earlier instructions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Instr {
    /// A constant, by its bits (so that `0.0` and `-0.0` stay distinct).
    Num(u64),
    X,
    Y,
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    Recip(u32),
    Pow(u32, u32),
    Powi(u32, i32),
    F1(Fn1, u32),
    F2(Fn2, u32, u32),
    Select([u32; 4]),
}

/// Expressions compiled together, with their common subexpressions computed once.
#[derive(Clone, Debug)]
pub struct ExprBatch {
    instrs: Vec<Instr>,
    outputs: Vec<u32>,
}

/// Working memory of [`ExprBatch::eval`]; one per thread, reused from call to call.
#[derive(Default)]
pub struct BatchScratch {
    slots: Vec<f64>,
}

struct Builder {
    instrs: Vec<Instr>,
    index: HashMap<Instr, u32>,
}

impl Builder {
    fn push(&mut self, ins: Instr) -> u32 {
        if let Some(&i) = self.index.get(&ins) {
            return i;
        }
        let i = u32::try_from(self.instrs.len()).expect("fewer than 2^32 instructions");
        self.instrs.push(ins);
        self.index.insert(ins, i);
        i
    }

    /// Lowers `n` exactly as `compile` orders its operations (n-ary sums and products as the
    /// left-to-right binary chain, literal integer exponents as `powi`).
    fn lower(&mut self, n: &Node) -> u32 {
        match n {
            Node::Num(v) => self.push(Instr::Num(v.to_bits())),
            Node::X => self.push(Instr::X),
            Node::Y => self.push(Instr::Y),
            Node::Neg(a) => {
                let a = self.lower(a);
                self.push(Instr::Neg(a))
            }
            Node::Sum(ts) | Node::Prod(ts) => {
                let is_sum = matches!(n, Node::Sum(_));
                let Some(((first_flag, first), rest)) = ts.split_first() else {
                    return self.push(Instr::Num(if is_sum { 0.0f64 } else { 1.0 }.to_bits()));
                };
                let mut acc = self.lower(first);
                if *first_flag {
                    acc = self.push(if is_sum {
                        Instr::Neg(acc)
                    } else {
                        Instr::Recip(acc)
                    });
                }
                for (flag, t) in rest {
                    let t = self.lower(t);
                    acc = self.push(match (is_sum, *flag) {
                        (true, false) => Instr::Add(acc, t),
                        (true, true) => Instr::Sub(acc, t),
                        (false, false) => Instr::Mul(acc, t),
                        (false, true) => Instr::Div(acc, t),
                    });
                }
                acc
            }
            Node::Pow(a, b) => {
                let a = self.lower(a);
                match literal_int(b) {
                    Some(k) => self.push(Instr::Powi(a, k)),
                    None => {
                        let b = self.lower(b);
                        self.push(Instr::Pow(a, b))
                    }
                }
            }
            Node::F1(f, a) => {
                let a = self.lower(a);
                self.push(Instr::F1(*f, a))
            }
            Node::F2(f, a, b) => {
                let a = self.lower(a);
                let b = self.lower(b);
                self.push(Instr::F2(*f, a, b))
            }
            Node::Select(s) => {
                let args = [0, 1, 2, 3].map(|k| self.lower(&s[k]));
                self.push(Instr::Select(args))
            }
        }
    }
}

impl ExprBatch {
    /// Compiles `exprs` together; [`ExprBatch::eval`] returns their values in this order.
    pub fn new(exprs: &[&Expr]) -> ExprBatch {
        let mut b = Builder {
            instrs: Vec::new(),
            index: HashMap::new(),
        };
        let outputs = exprs.iter().map(|e| b.lower(&e.inner.root)).collect();
        ExprBatch {
            instrs: b.instrs,
            outputs,
        }
    }

    /// Number of expressions.
    pub fn len(&self) -> usize {
        self.outputs.len()
    }

    /// True when compiled from no expression.
    pub fn is_empty(&self) -> bool {
        self.outputs.is_empty()
    }

    /// Number of distinct subexpressions (instructions) of the program.
    pub fn instructions(&self) -> usize {
        self.instrs.len()
    }

    /// Evaluates every expression at the points `(xs[j], ys[j])`: expression k's value at point j
    /// goes to `out[k * n + j]`, n = `xs.len()`. Panics when `ys` or `out` has the wrong length.
    pub fn eval(&self, xs: &[f64], ys: &[f64], scratch: &mut BatchScratch, out: &mut [f64]) {
        let n = xs.len();
        assert_eq!(ys.len(), n, "as many y as x");
        assert_eq!(
            out.len(),
            n * self.outputs.len(),
            "one value per expression and point"
        );
        scratch.slots.resize(self.instrs.len() * LANES, 0.0);
        for start in (0..n).step_by(LANES) {
            let m = LANES.min(n - start);
            self.run(
                &xs[start..start + m],
                &ys[start..start + m],
                &mut scratch.slots,
            );
            for (k, &o) in self.outputs.iter().enumerate() {
                let src = &scratch.slots[o as usize * LANES..][..m];
                out[k * n + start..][..m].copy_from_slice(src);
            }
        }
    }

    /// One pass over the program for m = `xs.len()` ≤ [`LANES`] points.
    fn run(&self, xs: &[f64], ys: &[f64], slots: &mut [f64]) {
        let m = xs.len();
        for (i, ins) in self.instrs.iter().enumerate() {
            let (done, rest) = slots.split_at_mut(i * LANES);
            let dst = &mut rest[..m];
            let arg = |k: u32| &done[k as usize * LANES..][..m];
            let unary = |dst: &mut [f64], a: u32, f: &dyn Fn(f64) -> f64| {
                for (d, &v) in dst.iter_mut().zip(arg(a)) {
                    *d = f(v);
                }
            };
            let binary = |dst: &mut [f64], a: u32, b: u32, f: &dyn Fn(f64, f64) -> f64| {
                for ((d, &u), &v) in dst.iter_mut().zip(arg(a)).zip(arg(b)) {
                    *d = f(u, v);
                }
            };
            match *ins {
                Instr::Num(bits) => dst.fill(f64::from_bits(bits)),
                Instr::X => dst.copy_from_slice(xs),
                Instr::Y => dst.copy_from_slice(ys),
                // The arithmetic loops are written out so that they vectorise.
                Instr::Add(a, b) => {
                    for ((d, &u), &v) in dst.iter_mut().zip(arg(a)).zip(arg(b)) {
                        *d = u + v;
                    }
                }
                Instr::Sub(a, b) => {
                    for ((d, &u), &v) in dst.iter_mut().zip(arg(a)).zip(arg(b)) {
                        *d = u - v;
                    }
                }
                Instr::Mul(a, b) => {
                    for ((d, &u), &v) in dst.iter_mut().zip(arg(a)).zip(arg(b)) {
                        *d = u * v;
                    }
                }
                Instr::Div(a, b) => {
                    for ((d, &u), &v) in dst.iter_mut().zip(arg(a)).zip(arg(b)) {
                        *d = u / v;
                    }
                }
                Instr::Neg(a) => {
                    for (d, &v) in dst.iter_mut().zip(arg(a)) {
                        *d = -v;
                    }
                }
                Instr::Recip(a) => {
                    for (d, &v) in dst.iter_mut().zip(arg(a)) {
                        *d = 1.0 / v;
                    }
                }
                Instr::Pow(a, b) => binary(dst, a, b, &f64::powf),
                Instr::Powi(a, k) => unary(dst, a, &|v| v.powi(k)),
                Instr::F1(f, a) => unary(dst, a, &|v| f.apply(v)),
                Instr::F2(f, a, b) => binary(dst, a, b, &|u, v| f.apply(u, v)),
                Instr::Select([a, b, c, e]) => {
                    let (a, b, c, e) = (arg(a), arg(b), arg(c), arg(e));
                    for j in 0..m {
                        dst[j] = if a[j] < b[j] { c[j] } else { e[j] };
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Var;

    const OPEN: &str =
        "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)";

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// Points on a grid through the crack line (signed zeros included) and off it.
    fn points() -> (Vec<f64>, Vec<f64>) {
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for i in 0..23 {
            for (j, y) in [-0.7, -0.25, -0.0, 0.0, 1e-9, 0.3, 0.999]
                .into_iter()
                .enumerate()
            {
                xs.push(-1.0 + 2.0 * i as f64 / 22.0 + 1e-3 * j as f64);
                ys.push(y);
            }
        }
        (xs, ys)
    }

    #[test]
    fn values_are_those_of_the_stack_program_bit_for_bit() {
        let sources = [
            OPEN,
            "20*sin(2*pi*x)*sign(y)",
            "min(x, y) * max(x, 2*y) - abs(x - y)",
            "exp(-x*x) * cos(y) + log(1 + x^2) / sqrt(2 + y^2) + tan(x/3)",
            "(x+1)^0.5 + 2^x - x^-3 + y^2",
            "-x/y/2 + 1/(x - y)",
        ];
        let mut exprs: Vec<Expr> = Vec::new();
        for s in sources {
            let e = Expr::parse(s).expect("valid");
            exprs.push(e.derivative(Var::X));
            exprs.push(e.derivative(Var::Y).derivative(Var::X));
            exprs.push(e);
        }
        let refs: Vec<&Expr> = exprs.iter().collect();
        let batch = ExprBatch::new(&refs);
        assert_eq!(batch.len(), exprs.len());
        let (xs, ys) = points();
        assert!(xs.len() > 2 * LANES, "several passes, the last one partial");
        let n = xs.len();
        let mut out = vec![0.0; n * batch.len()];
        batch.eval(&xs, &ys, &mut BatchScratch::default(), &mut out);
        for (k, e) in exprs.iter().enumerate() {
            for j in 0..n {
                let (got, want) = (out[k * n + j], e.eval(xs[j], ys[j]));
                assert!(
                    same(got, want),
                    "{} at ({}, {}): batch {got:e}, stack {want:e}",
                    e.source(),
                    xs[j],
                    ys[j]
                );
            }
        }
    }

    /// u and its derivatives share their subexpressions: u = sqrt(sqrt(P)) · sin(Q) costs one
    /// instruction (the product) once ∂u/∂x and ∂u/∂y, which contain both factors, are computed.
    #[test]
    fn common_subexpressions_are_computed_once() {
        let u = Expr::parse(OPEN).expect("valid");
        let (px, py) = (u.derivative(Var::X), u.derivative(Var::Y));
        let derivatives = ExprBatch::new(&[&px, &py]).instructions();
        let together = ExprBatch::new(&[&u, &px, &py]).instructions();
        assert_eq!(together, derivatives + 1);
        // x, 1, x + 1, (x + 1)(x + 1)
        let square = Expr::parse("(x+1)*(x+1)").expect("valid");
        assert_eq!(ExprBatch::new(&[&square]).instructions(), 4);
        // 0.0 and -0.0 are different constants
        let z = ExprBatch::new(&[&Expr::constant(0.0), &Expr::constant(-0.0)]);
        let mut out = [1.0; 2];
        z.eval(&[0.5], &[0.5], &mut BatchScratch::default(), &mut out);
        assert!(out[0].is_sign_positive() && out[1].is_sign_negative());
    }
}
