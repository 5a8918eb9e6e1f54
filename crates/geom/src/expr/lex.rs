//! Splitting expression text into tokens.
//!
//! Invariants:
//! - Every token's span is a byte range on char boundaries of the input, so error spans can
//!   always be sliced out of the text.
//! - Lexing never fails as a whole: a malformed number or a stray character becomes an
//!   [`Tok::Bad`] token carrying its error. The parser reports it only when it reaches it, so
//!   the leftmost problem in the text is the one reported.

use std::ops::Range;

use super::ParseError;

#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok {
    Num(f64),
    Ident,
    Plus,
    Minus,
    Star,
    /// `**`: not an operator of the language, but common enough to deserve its own help.
    StarStar,
    Slash,
    Caret,
    LParen,
    RParen,
    Comma,
    Bad(Box<ParseError>),
    End,
}

#[derive(Clone, Debug)]
pub(crate) struct Token {
    pub tok: Tok,
    pub span: Range<usize>,
}

/// Tokens of `text`, always ending with [`Tok::End`] (span `len..len`).
pub(crate) fn tokenize(text: &str) -> Vec<Token> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        let start = i;
        let single = match b {
            b'+' => Some(Tok::Plus),
            b'-' => Some(Tok::Minus),
            b'/' => Some(Tok::Slash),
            b'^' => Some(Tok::Caret),
            b'(' => Some(Tok::LParen),
            b')' => Some(Tok::RParen),
            b',' => Some(Tok::Comma),
            _ => None,
        };
        if let Some(tok) = single {
            i += 1;
            out.push(Token {
                tok,
                span: start..i,
            });
        } else if b == b'*' {
            if bytes.get(i + 1) == Some(&b'*') {
                i += 2;
                out.push(Token {
                    tok: Tok::StarStar,
                    span: start..i,
                });
            } else {
                i += 1;
                out.push(Token {
                    tok: Tok::Star,
                    span: start..i,
                });
            }
        } else if b.is_ascii_whitespace() {
            i += 1;
        } else if b.is_ascii_digit() || b == b'.' {
            i = number_end(bytes, i);
            out.push(Token {
                tok: number(&text[start..i], start..i),
                span: start..i,
            });
        } else if b.is_ascii_alphabetic() || b == b'_' {
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            out.push(Token {
                tok: Tok::Ident,
                span: start..i,
            });
        } else {
            // Step over the whole character so the span stays on char boundaries.
            let ch = text[start..].chars().next().unwrap_or('\u{fffd}');
            i += ch.len_utf8().max(1);
            let error = ParseError {
                span: start..i,
                message: format!("unexpected character `{ch}`"),
                help: None,
            };
            out.push(Token {
                tok: Tok::Bad(Box::new(error)),
                span: start..i,
            });
        }
    }
    out.push(Token {
        tok: Tok::End,
        span: text.len()..text.len(),
    });
    out
}

fn is_word_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'.'
}

/// End of the number-like run starting at `i`. The run is deliberately greedy (letters, dots,
/// and a sign right after an exponent letter) so that `1.2.3` or `2x` is reported as one bad
/// number rather than as two puzzling tokens.
fn number_end(bytes: &[u8], mut i: usize) -> usize {
    while i < bytes.len() {
        let b = bytes[i];
        let after_exponent = i > 0 && matches!(bytes[i - 1], b'e' | b'E');
        if is_word_byte(b) || (after_exponent && matches!(b, b'+' | b'-')) {
            i += 1;
        } else {
            break;
        }
    }
    i
}

fn number(run: &str, span: Range<usize>) -> Tok {
    let bad = |message: String, help: Option<String>| {
        Tok::Bad(Box::new(ParseError {
            span: span.clone(),
            message,
            help,
        }))
    };
    // The run starts with a digit or '.', so `f64::from_str` cannot see a sign, `inf` or `nan`.
    match run.parse::<f64>() {
        Ok(v) if v.is_finite() => Tok::Num(v),
        Ok(_) => bad(format!("number `{run}` is too large"), None),
        Err(_) => {
            let help = implicit_product(run).map(|(num, name)| {
                format!("multiplication needs an explicit `*`: write `{num}*{name}`")
            });
            bad(format!("invalid number `{run}`"), help)
        }
    }
}

/// Splits `2x` / `3pi` into the number and the name written right after it, if that is what
/// the run looks like.
fn implicit_product(run: &str) -> Option<(&str, &str)> {
    let letter = run.find(|c: char| c.is_ascii_alphabetic())?;
    // An exponent letter belongs to the number when digits follow it (`2e5x` → `2e5`, `x`).
    let mut split = letter;
    let rest = &run[letter..];
    if rest.starts_with(['e', 'E']) {
        let digits = rest[1..].trim_start_matches(['+', '-']);
        let exp_len = digits.len()
            - digits
                .trim_start_matches(|c: char| c.is_ascii_digit())
                .len();
        if exp_len > 0 {
            split = run.len() - digits.len() + exp_len;
        }
    }
    let (num, name) = run.split_at(split);
    let name_ok = name.starts_with(|c: char| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    (num.parse::<f64>().is_ok() && name_ok).then_some((num, name))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> Vec<Tok> {
        tokenize(text).into_iter().map(|t| t.tok).collect()
    }

    #[test]
    fn numbers_in_every_spelling() {
        for (text, value) in [
            ("1", 1.0),
            ("0.5", 0.5),
            (".5", 0.5),
            ("1e-3", 1e-3),
            ("2.5E+2", 250.0),
            ("3.", 3.0),
        ] {
            assert_eq!(kinds(text), vec![Tok::Num(value), Tok::End], "{text}");
        }
    }

    #[test]
    fn spans_are_byte_ranges() {
        let spans: Vec<_> = tokenize(" sin( x )**2")
            .into_iter()
            .map(|t| t.span)
            .collect();
        assert_eq!(spans, vec![1..4, 4..5, 6..7, 8..9, 9..11, 11..12, 12..12]);
    }

    #[test]
    fn implicit_products_are_recognised() {
        assert_eq!(implicit_product("2x"), Some(("2", "x")));
        assert_eq!(implicit_product("2e5x"), Some(("2e5", "x")));
        assert_eq!(implicit_product("3pi"), Some(("3", "pi")));
        assert_eq!(implicit_product("2e"), Some(("2", "e")));
        assert_eq!(implicit_product("1.2.3"), None);
        assert_eq!(implicit_product("1_000"), None);
    }
}
