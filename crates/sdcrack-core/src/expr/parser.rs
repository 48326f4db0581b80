//! The recursive-descent parser of the grammar in the [module documentation](super): tokens to
//! the expression tree, with the length and nesting limits, and a "did you mean" suggestion
//! for a misspelt function or variable name.

use super::error::{ExprError, MAX_DEPTH, MAX_LEN};
use super::lexer::{lex, Tok, Token};
use super::tree::{Fn1, Fn2, Node};

pub(super) fn parse_src(src: &str) -> Result<Node, ExprError> {
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

pub(super) struct Parser {
    toks: Vec<Token>,
    pos: usize,
    depth: usize,
}

pub(super) const FUNC_NAMES: [&str; 11] = [
    "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sign", "atan2", "min", "max",
];

/// The closest candidate for a near-miss name by plain Levenshtein distance (insertions,
/// deletions, substitutions; no transpositions), first in list order on ties.
pub(super) fn suggest(name: &str, candidates: &[&'static str]) -> Option<&'static str> {
    if name.len() > 12 {
        return None;
    }
    let lower = name.to_ascii_lowercase();
    let mut best: Option<(usize, &'static str)> = None;
    for &c in candidates {
        let d = strsim::levenshtein(&lower, c);
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

    /// A sum: terms joined by `+` and `−` (a lone term is itself).
    fn parse_expr(&mut self) -> Result<Node, ExprError> {
        self.parse_chain([Tok::Plus, Tok::Minus], Self::parse_term, Node::Sum)
    }

    /// A product: factors joined by `*` and `/` (a lone factor is itself).
    fn parse_term(&mut self) -> Result<Node, ExprError> {
        self.parse_chain([Tok::Star, Tok::Slash], Self::parse_unary, Node::Prod)
    }

    /// A left-associative chain `operand (op operand)*` of one precedence level whose operators
    /// are `[direct, inverse]` (`+`/`−`, `*`/`/`): a lone operand is returned as it is, two or
    /// more become `chain` of the operands in order, each flagged `true` after the inverse
    /// operator (the first `false`).
    fn parse_chain(
        &mut self,
        [direct, inverse]: [Tok; 2],
        operand: fn(&mut Self) -> Result<Node, ExprError>,
        chain: fn(Vec<(bool, Node)>) -> Node,
    ) -> Result<Node, ExprError> {
        let first = operand(self)?;
        let mut rest = Vec::new();
        loop {
            let inverted = match &self.peek().tok {
                t if *t == direct => false,
                t if *t == inverse => true,
                _ => break,
            };
            self.advance();
            rest.push((inverted, operand(self)?));
        }
        if rest.is_empty() {
            Ok(first)
        } else {
            rest.insert(0, (false, first));
            Ok(chain(rest))
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
