//! The expression lexer: characters to tokens (numbers, names, operators, parentheses,
//! commas), each token with the character position it starts at, for error messages.

use super::error::ExprError;

#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
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
pub(super) struct Token {
    pub(super) tok: Tok,
    pub(super) col: usize,
    pub(super) text: String,
}

pub(super) fn lex(chars: &[char]) -> Vec<Token> {
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
