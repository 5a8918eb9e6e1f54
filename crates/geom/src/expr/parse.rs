//! Recursive-descent parser from text to [`Expr`].
//!
//! Grammar (loosest first):
//! ```text
//! sum     = product (("+" | "-") product)*          left-associative
//! product = unary (("*" | "/") unary)*              left-associative
//! unary   = ("-" | "+") unary | power
//! power   = primary ("^" unary)?                    right-associative: 2^3^2 = 2^9
//! primary = number | name | name "(" sum ("," sum)* ")" | "(" sum ")"
//! ```
//! `^` binds tighter than unary minus (`-x^2 = -(x^2)`) but its exponent may carry one
//! (`2^-1`).
//!
//! Invariants:
//! - `parse` never panics and never overflows the stack: its recursion is capped at
//!   [`MAX_NESTING`] and the tree height at [`MAX_HEIGHT`], which also bounds every later
//!   recursive pass over the tree.
//! - Errors point at the leftmost problem; spans are byte ranges on char boundaries.
//! - Messages are lower case with names in backticks; `help` says how to fix it when we can.

use std::ops::Range;

use super::ParseError;
use super::ast::{BinOp, CONSTANTS, Expr, Func, Var};
use super::lex::{Tok, Token, tokenize};
use crate::spelling::closest;

/// Deepest nesting of parentheses, unary signs, powers and calls accepted. The parser
/// recurses through several frames per level, so this is kept well below [`MAX_HEIGHT`].
pub const MAX_NESTING: usize = 256;

/// Tallest tree accepted. Long sums are left-deep chains, so this is also the longest sum
/// without parentheses. Generous for hand-written formulas, and small enough that the
/// recursive passes over the tree fit comfortably in a 2 MiB thread stack.
pub const MAX_HEIGHT: usize = 1024;

const OPERAND_HELP: &str = "expected a number, a variable, a function call or `(`";
const VARIABLE_NAMES: [&str; 6] = ["x", "y", "z", "pi", "tau", "e"];
const FUNCTION_NAMES: [&str; 9] = [
    "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "min", "max",
];

/// Parses an expression in `x`, `y`, `z`. The tree is returned as written (no folding).
pub fn parse(text: &str) -> Result<Expr, ParseError> {
    let mut parser = Parser {
        text,
        toks: tokenize(text),
        pos: 0,
        depth: 0,
        open_parens: 0,
    };
    if parser.peek().tok == Tok::End {
        return Err(error(
            0..text.len(),
            "empty expression".into(),
            Some(OPERAND_HELP.into()),
        ));
    }
    let (expr, _) = parser.sum()?;
    let tok = parser.next();
    match tok.tok {
        Tok::End => Ok(expr),
        Tok::RParen => Err(error(tok.span, "unmatched `)`".into(), None)),
        _ => Err(parser.unexpected(tok, "expected an operator or the end of the expression")),
    }
}

/// A parsed subtree and its height (a leaf has height 1).
type Node = (Expr, usize);

struct Parser<'a> {
    text: &'a str,
    toks: Vec<Token>,
    pos: usize,
    depth: usize,
    open_parens: usize,
}

fn error(span: Range<usize>, message: String, help: Option<String>) -> ParseError {
    ParseError {
        span,
        message,
        help,
    }
}

impl Parser<'_> {
    fn peek(&self) -> &Token {
        // `tokenize` always ends with `End`, and `next` never steps past it.
        &self.toks[self.pos.min(self.toks.len() - 1)]
    }

    fn next(&mut self) -> Token {
        let tok = self.peek().clone();
        if tok.tok != Tok::End {
            self.pos += 1;
        }
        tok
    }

    fn slice(&self, span: &Range<usize>) -> &str {
        self.text.get(span.clone()).unwrap_or("")
    }

    fn enter(&mut self, span: &Range<usize>) -> Result<(), ParseError> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(too_deep(span.clone()));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    /// An error for a token that cannot stand where it is. A malformed token reports its own
    /// error instead, since that is the real problem.
    fn unexpected(&self, tok: Token, expected: &str) -> ParseError {
        let help = Some(expected.to_string());
        match tok.tok {
            Tok::Bad(e) => *e,
            Tok::End => error(tok.span, "unexpected end of input".into(), help),
            Tok::StarStar => error(
                tok.span,
                "unexpected `**`".into(),
                Some("write powers with `^`, e.g. `x^2`".into()),
            ),
            _ => {
                let message = format!("unexpected `{}`", self.slice(&tok.span));
                error(tok.span, message, help)
            }
        }
    }

    fn sum(&mut self) -> Result<Node, ParseError> {
        let mut lhs = self.product()?;
        loop {
            let op = match self.peek().tok {
                Tok::Plus => BinOp::Add,
                Tok::Minus => BinOp::Sub,
                _ => return Ok(lhs),
            };
            let span = self.next().span;
            let rhs = self.product()?;
            lhs = join(op, lhs, rhs, span)?;
        }
    }

    fn product(&mut self) -> Result<Node, ParseError> {
        let mut lhs = self.unary()?;
        loop {
            let op = match self.peek().tok {
                Tok::Star => BinOp::Mul,
                Tok::Slash => BinOp::Div,
                _ => return Ok(lhs),
            };
            let span = self.next().span;
            let rhs = self.unary()?;
            lhs = join(op, lhs, rhs, span)?;
        }
    }

    fn unary(&mut self) -> Result<Node, ParseError> {
        let negate = match self.peek().tok {
            Tok::Minus => true,
            Tok::Plus => false,
            _ => return self.power(),
        };
        let span = self.next().span;
        self.enter(&span)?;
        let (operand, height) = self.unary()?;
        self.leave();
        if !negate {
            return Ok((operand, height));
        }
        if height + 1 > MAX_HEIGHT {
            return Err(too_tall(span));
        }
        Ok((Expr::Neg(Box::new(operand)), height + 1))
    }

    fn power(&mut self) -> Result<Node, ParseError> {
        let base = self.primary()?;
        if self.peek().tok != Tok::Caret {
            return Ok(base);
        }
        let span = self.next().span;
        self.enter(&span)?;
        let exponent = self.unary()?;
        self.leave();
        join(BinOp::Pow, base, exponent, span)
    }

    fn primary(&mut self) -> Result<Node, ParseError> {
        let tok = self.next();
        match tok.tok {
            Tok::Num(v) => Ok((Expr::Num(v), 1)),
            Tok::Ident if self.peek().tok == Tok::LParen => self.call(tok.span),
            Tok::Ident => self.name(tok.span),
            Tok::LParen => {
                self.enter(&tok.span)?;
                self.open_parens += 1;
                let inner = self.sum()?;
                self.close(tok.span, "expected an operator or `)`")?;
                self.open_parens -= 1;
                self.leave();
                Ok(inner)
            }
            Tok::RParen if self.open_parens == 0 => {
                Err(error(tok.span, "unmatched `)`".into(), None))
            }
            _ => Err(self.unexpected(tok, OPERAND_HELP)),
        }
    }

    /// Consumes the `)` closing the `(` at `open`, returning its span.
    fn close(&mut self, open: Range<usize>, expected: &str) -> Result<Range<usize>, ParseError> {
        let tok = self.next();
        match tok.tok {
            Tok::RParen => Ok(tok.span),
            Tok::End => Err(error(
                open,
                "unclosed `(`".into(),
                Some("add a matching `)`".into()),
            )),
            _ => Err(self.unexpected(tok, expected)),
        }
    }

    /// A variable or constant.
    fn name(&mut self, span: Range<usize>) -> Result<Node, ParseError> {
        let name = self.slice(&span);
        let var = Var::ALL.into_iter().find(|v| v.name() == name);
        if let Some(v) = var {
            return Ok((Expr::Var(v), 1));
        }
        if let Some((_, value)) = CONSTANTS.iter().find(|(n, _)| *n == name) {
            return Ok((Expr::Num(*value), 1));
        }
        if FUNCTION_NAMES.contains(&name) {
            let message = format!("function `{name}` needs its arguments in parentheses");
            return Err(error(span, message, Some(format!("write `{name}(...)`"))));
        }
        let message = format!(
            "unknown variable `{name}`: the available names are `x`, `y`, `z`, `pi`, `tau` and `e`"
        );
        Err(error(span, message, suggestion(name, &VARIABLE_NAMES)))
    }

    /// A function call; the current token is its `(`.
    fn call(&mut self, name_span: Range<usize>) -> Result<Node, ParseError> {
        let name = self.slice(&name_span).to_string();
        enum Kind {
            One(Func),
            Many(BinOp),
        }
        let kind = match name.as_str() {
            "min" => Kind::Many(BinOp::Min),
            "max" => Kind::Many(BinOp::Max),
            _ => match Func::ALL.into_iter().find(|f| f.name() == name) {
                Some(f) => Kind::One(f),
                None if VARIABLE_NAMES.contains(&name.as_str()) => {
                    let message = format!("`{name}` is not a function");
                    let help =
                        format!("multiplication needs an explicit `*`: write `{name}*(...)`");
                    return Err(error(name_span, message, Some(help)));
                }
                None => {
                    let message = format!("unknown function `{name}`");
                    let help = suggestion(&name, &FUNCTION_NAMES).or_else(|| {
                        Some(format!(
                            "the available functions are {}",
                            FUNCTION_NAMES.map(|f| format!("`{f}`")).join(", ")
                        ))
                    });
                    return Err(error(name_span, message, help));
                }
            },
        };

        let open = self.next().span;
        self.enter(&open)?;
        self.open_parens += 1;
        let mut args: Vec<Node> = Vec::new();
        let close = if self.peek().tok == Tok::RParen {
            self.next().span
        } else {
            loop {
                args.push(self.sum()?);
                if self.peek().tok == Tok::Comma {
                    self.next();
                    continue;
                }
                break self.close(open.clone(), "expected an operator, `,` or `)`")?;
            }
        };
        self.open_parens -= 1;
        self.leave();

        let call_span = name_span.start..close.end;
        let given = args.len();
        match kind {
            Kind::One(f) => {
                let mut args = args.into_iter();
                match (args.next(), args.next()) {
                    (Some((arg, height)), None) => {
                        if height + 1 > MAX_HEIGHT {
                            return Err(too_tall(call_span));
                        }
                        Ok((Expr::call(f, arg), height + 1))
                    }
                    _ => Err(error(
                        call_span,
                        format!("`{name}` takes 1 argument but was given {given}"),
                        None,
                    )),
                }
            }
            Kind::Many(op) => {
                let mut args = args.into_iter();
                let (Some(first), Some(second)) = (args.next(), args.next()) else {
                    return Err(error(
                        call_span,
                        format!("`{name}` takes at least 2 arguments but was given {given}"),
                        None,
                    ));
                };
                let mut acc = join(op, first, second, call_span.clone())?;
                for arg in args {
                    acc = join(op, acc, arg, call_span.clone())?;
                }
                Ok(acc)
            }
        }
    }
}

fn join(op: BinOp, (a, ha): Node, (b, hb): Node, span: Range<usize>) -> Result<Node, ParseError> {
    let height = ha.max(hb) + 1;
    if height > MAX_HEIGHT {
        return Err(too_tall(span));
    }
    Ok((Expr::binary(op, a, b), height))
}

fn too_deep(span: Range<usize>) -> ParseError {
    error(
        span,
        "expression is nested too deeply".into(),
        Some(format!(
            "at most {MAX_NESTING} levels of parentheses, signs, powers and calls are supported"
        )),
    )
}

fn too_tall(span: Range<usize>) -> ParseError {
    error(
        span,
        "expression is nested too deeply".into(),
        Some(format!(
            "at most {MAX_HEIGHT} chained operations are supported; group long sums in parentheses"
        )),
    )
}

/// "did you mean" help. A one-letter name is close to every other one-letter name, so for
/// those only a difference of case counts as a likely typo (`X` → `x`, but not `w` → `x`).
fn suggestion(name: &str, candidates: &[&'static str]) -> Option<String> {
    let best = if name.chars().count() == 1 {
        candidates
            .iter()
            .copied()
            .find(|c| c.eq_ignore_ascii_case(name))
    } else {
        closest(name, candidates.iter().copied())
    };
    best.map(|c| format!("did you mean `{c}`?"))
}
