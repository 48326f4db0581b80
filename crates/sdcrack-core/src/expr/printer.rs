//! Rendering the expression tree back to text that [`Expr::parse`](super::Expr::parse)
//! accepts: numbers in their shortest round-trip form, every operator application wrapped
//! in parentheses.

use super::tree::Node;

pub(super) fn render_root(n: &Node) -> String {
    let mut out = String::new();
    render(n, &mut out, true);
    out
}

pub(super) fn render_num(v: f64, out: &mut String) {
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
pub(super) fn render(n: &Node, out: &mut String, wrap: bool) {
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
