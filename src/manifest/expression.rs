//! Checking `expr = "…"` formulas and mapping the parser's errors into the manifest.
//!
//! Invariant: an expression error is shown at the exact character of the TOML file (or `--set`
//! argument) it concerns whenever the string's source text equals its value (a basic string
//! without escapes, a literal string, or a raw `--set` value); otherwise the whole string is
//! underlined, since offsets in the decoded value no longer match the file.

use std::ops::Range;

use latticebuild_geom::expr::ParseError;

use super::source::Sources;
use crate::diagnostics::Diagnostic;

/// Checks an expression's syntax and names with the geometry crate's parser (an empty formula
/// gets its own, friendlier message).
pub(crate) fn check_expression(text: &str) -> Result<(), ParseError> {
    if text.trim().is_empty() {
        return Err(ParseError {
            span: 0..text.len(),
            message: "empty expression".to_string(),
            help: Some("write a formula in x, y and z, e.g. `cos(x) + cos(y) + cos(z)`".into()),
        });
    }
    latticebuild_geom::expr::parse(text).map(|_| ())
}

/// The diagnostic for an expression error in the string value at `value_span` (`key` names it,
/// e.g. `cells.a.expr`), and the span it cites.
pub(crate) fn error_at(
    sources: &Sources<'_>,
    key: &str,
    value_span: &Range<usize>,
    value: &str,
    err: ParseError,
) -> (Range<usize>, Diagnostic) {
    let span = match content_start(sources, value_span, value) {
        Some(start) => {
            // Clamped so that a parser reporting a span past the end cannot point elsewhere.
            let from = err.span.start.min(value.len());
            let to = err.span.end.clamp(from, value.len());
            start + from..start + to
        }
        None => value_span.clone(),
    };
    let mut diag =
        Diagnostic::error(format!("invalid expression in `{key}`")).with_label(err.message);
    if let Some(help) = err.help {
        diag = diag.with_help(help);
    }
    (span, diag)
}

/// Where the characters of `value` start in the source, if the source spells them unchanged.
pub(crate) fn content_start(
    sources: &Sources<'_>,
    span: &Range<usize>,
    value: &str,
) -> Option<usize> {
    let raw = sources.slice(span)?;
    if raw == value {
        return Some(span.start);
    }
    let single_quoted = |q: &str| {
        raw.len() >= 2 && raw.starts_with(q) && raw.ends_with(q) && !raw.starts_with(&q.repeat(3))
    };
    if (single_quoted("\"") || single_quoted("'")) && raw.get(1..raw.len() - 1) == Some(value) {
        return Some(span.start + 1);
    }
    None
}
