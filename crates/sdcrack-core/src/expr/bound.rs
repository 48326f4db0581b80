//! Evaluation with a running round-off bound: the value of an expression at a point together
//! with a first-order bound of its floating-point error (Wilkinson's running error analysis,
//! Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., §3.3). The point's
//! coordinates are taken as exact; every operation adds its own rounding (`U`·|result| for the
//! correctly rounded `+ − × ÷ √`, `2U`·|result| for the libm functions, which are within one ulp)
//! to the errors of its operands propagated through its derivative. A decision that the
//! operands' errors could flip (`sign` of a value within its error of 0, the branch of `atan2`
//! on its cut, a `min`/`max` selection of a derivative) adds the largest change it can make. The
//! bound is what the scene's exact-data check ([`crate::scene::exact_data`]) uses as the
//! round-off tolerance of two values that should agree.

use super::tree::{Fn1, Fn2};
use super::vm::Op;

/// The unit round-off of f64, 2⁻⁵³.
const U: f64 = f64::EPSILON / 2.0;

/// `coefficient · error` with 0 · ∞ = 0: an operand without error contributes none, however
/// sensitive the operation is to it.
fn scaled(coefficient: f64, error: f64) -> f64 {
    if error == 0.0 {
        0.0
    } else {
        coefficient.abs() * error
    }
}

/// Runs `code` at (x, y) on a stack of (value, error bound) pairs.
pub(super) fn run_bounded(code: &[Op], x: f64, y: f64) -> (f64, f64) {
    let mut st: Vec<(f64, f64)> = Vec::with_capacity(16);
    for op in code {
        match *op {
            // an integer literal is exact; others (0.1, pi) are rounded
            Op::Num(v) => st.push((v, if v.fract() == 0.0 { 0.0 } else { U * v.abs() })),
            Op::X => st.push((x, 0.0)),
            Op::Y => st.push((y, 0.0)),
            Op::Neg => {
                let (a, ea) = st.pop().expect("operand");
                st.push((-a, ea));
            }
            Op::Recip => {
                let (a, ea) = st.pop().expect("operand");
                let v = 1.0 / a;
                st.push((v, scaled(v / a, ea) + U * v.abs()));
            }
            Op::Powi(k) => {
                let (a, ea) = st.pop().expect("operand");
                let v = a.powi(k);
                // powi multiplies |k| times at most (then one division for k < 0)
                let roundings = f64::from(k.unsigned_abs().max(1)) + 1.0;
                let slope = f64::from(k) * a.powi(k - 1);
                st.push((v, scaled(slope, ea) + roundings * U * v.abs()));
            }
            Op::F1(f) => {
                let (a, ea) = st.pop().expect("operand");
                st.push(fn1_bounded(f, a, ea));
            }
            Op::Select => {
                let (d, ed) = st.pop().expect("operand");
                let (c, ec) = st.pop().expect("operand");
                let (b, eb) = st.pop().expect("operand");
                let (a, ea) = st.pop().expect("operand");
                let (v, e) = if a < b { (c, ec) } else { (d, ed) };
                // the comparison may go either way within the operands' errors
                let undecided = (a - b).abs() <= ea + eb && ea + eb > 0.0;
                let flip = if undecided {
                    ec.max(ed) + (c - d).abs()
                } else {
                    e
                };
                st.push((v, flip));
            }
            Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Pow | Op::F2(_) => {
                let (b, eb) = st.pop().expect("operand");
                let (a, ea) = st.pop().expect("operand");
                st.push(binary_bounded(op, (a, ea), (b, eb)));
            }
        }
    }
    st.pop().unwrap_or((f64::NAN, f64::INFINITY))
}

fn binary_bounded(op: &Op, (a, ea): (f64, f64), (b, eb): (f64, f64)) -> (f64, f64) {
    match *op {
        Op::Add => {
            let v = a + b;
            (v, ea + eb + U * v.abs())
        }
        Op::Sub => {
            let v = a - b;
            (v, ea + eb + U * v.abs())
        }
        Op::Mul => {
            let v = a * b;
            (v, scaled(b, ea) + scaled(a, eb) + U * v.abs())
        }
        Op::Div => {
            let v = a / b;
            (v, scaled(1.0 / b, ea) + scaled(v / b, eb) + U * v.abs())
        }
        Op::Pow => {
            let v = a.powf(b);
            let da = b * a.powf(b - 1.0);
            let db = if v == 0.0 { 0.0 } else { v * a.abs().ln() }; // 0^b: flat in b > 0
            (v, scaled(da, ea) + scaled(db, eb) + 2.0 * U * v.abs())
        }
        Op::F2(Fn2::Atan2) => {
            let v = a.atan2(b);
            let r2 = a * a + b * b;
            let mut e = scaled(b / r2, ea) + scaled(a / r2, eb) + 2.0 * U * v.abs();
            // on the branch cut (b < 0, a within its error of 0) the angle may jump by 2π
            if b < 0.0 && a.abs() <= ea && ea > 0.0 {
                e += 2.0 * std::f64::consts::PI;
            }
            (v, e)
        }
        Op::F2(f) => (f.apply(a, b), ea.max(eb)), // min and max: 1-Lipschitz in each operand
        _ => unreachable!("binary operations only"),
    }
}

fn fn1_bounded(f: Fn1, a: f64, ea: f64) -> (f64, f64) {
    let v = f.apply(a);
    let libm = 2.0 * U * v.abs();
    let e = match f {
        Fn1::Sin => scaled(a.cos(), ea) + libm,
        Fn1::Cos => scaled(a.sin(), ea) + libm,
        Fn1::Tan => scaled(1.0 / (a.cos() * a.cos()), ea) + libm,
        Fn1::Exp => scaled(v, ea) + libm,
        Fn1::Log => scaled(1.0 / a, ea) + libm,
        Fn1::Sqrt => scaled(0.5 / v, ea) + U * v.abs(),
        Fn1::Abs => ea,
        // sign(a) may be either sign when a is within its error of 0: a change of 2 at most
        Fn1::Sign => {
            if ea > 0.0 && a.abs() <= ea {
                2.0
            } else {
                0.0
            }
        }
    };
    (v, e)
}
